//! Shards: a fixed mapping from units to tasks, so any task can be rerun alone and every unit
//! belongs to exactly one task. Of `U` units, unit `u` sits at position `p = u k mod U` of a
//! fixed scrambled order (`k` coprime to `U`, near `0.618 U`: neighbouring units land far
//! apart) and task `I` of `N` takes the block of positions `[I U / N, (I + 1) U / N)`.
//! Plain striding (`u mod N`) would give each task whole columns of tiles when `N` divides
//! the grid's columns, and the costly middle columns to a few tasks. The defaults come
//! from a Slurm array (`SLURM_ARRAY_TASK_ID` minus `SLURM_ARRAY_TASK_MIN`, and
//! `SLURM_ARRAY_TASK_COUNT`); Kubernetes indexed jobs and AWS Batch arrays pass
//! `--shard $JOB_COMPLETION_INDEX/N` or `--shard $AWS_BATCH_JOB_ARRAY_INDEX/N`.

use crate::error::FarmError;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// Most shards of one job.
pub const MAX_SHARDS: usize = 1_000_000;

/// Task `index` of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// This task's index, in `0..count`.
    pub index: usize,
    /// Tasks in the array, [1, [`MAX_SHARDS`]].
    pub count: usize,
}

impl Shard {
    /// The whole job in one task.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// A checked shard.
    pub fn new(index: usize, count: usize) -> Result<Shard, FarmError> {
        if count == 0 || count > MAX_SHARDS {
            return Err(FarmError::ShardCount {
                count,
                max: MAX_SHARDS,
            });
        }
        if index >= count {
            return Err(FarmError::ShardOutOfRange { index, count });
        }
        Ok(Shard { index, count })
    }

    /// Whether unit `u` of `total` belongs to this shard.
    pub fn owns(&self, u: usize, total: usize) -> bool {
        (position(u, total) as u128 * self.count as u128 / total.max(1) as u128) as usize
            == self.index
    }

    /// The units of this shard among `total`, in increasing order.
    pub fn units(&self, total: usize) -> Vec<usize> {
        (0..total).filter(|&u| self.owns(u, total)).collect()
    }

    /// The shard a Slurm array task is, from its environment (`None` outside an array).
    pub fn from_env() -> Result<Option<Shard>, FarmError> {
        Shard::from_vars(|k| std::env::var(k).ok())
    }

    /// [`Shard::from_env`] over any variable lookup (for tests).
    pub fn from_vars(var: impl Fn(&str) -> Option<String>) -> Result<Option<Shard>, FarmError> {
        let num = |name: &'static str| -> Result<Option<usize>, FarmError> {
            match var(name) {
                None => Ok(None),
                Some(v) => v
                    .trim()
                    .parse::<usize>()
                    .map(Some)
                    .map_err(|_| FarmError::Env {
                        name,
                        value: v.clone(),
                        why: "not a whole number".into(),
                    }),
            }
        };
        let Some(id) = num("SLURM_ARRAY_TASK_ID")? else {
            return Ok(None);
        };
        let Some(count) = num("SLURM_ARRAY_TASK_COUNT")? else {
            return Err(FarmError::Env {
                name: "SLURM_ARRAY_TASK_COUNT",
                value: String::new(),
                why: "SLURM_ARRAY_TASK_ID is set but the task count is not; pass --shard I/N"
                    .into(),
            });
        };
        let min = num("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
        let index = id.checked_sub(min).ok_or(FarmError::Env {
            name: "SLURM_ARRAY_TASK_ID",
            value: id.to_string(),
            why: format!("below SLURM_ARRAY_TASK_MIN={min}"),
        })?;
        Shard::new(index, count).map(Some)
    }
}

/// Unit `u`'s position in the fixed scrambled order of `total` units.
fn position(u: usize, total: usize) -> usize {
    let k = scramble(total) as u128;
    ((u as u128 * k) % total.max(1) as u128) as usize
}

/// The multiplier of [`position`]: the first number from `0.618 total` up that is coprime to
/// `total` (1 for one or two units).
fn scramble(total: usize) -> usize {
    fn gcd(a: usize, b: usize) -> usize {
        if b == 0 { a } else { gcd(b, a % b) }
    }
    if total <= 2 {
        return 1;
    }
    let mut k = ((total as f64 * 0.618_033_988_75) as usize).max(1);
    while gcd(k, total) != 1 {
        k += 1;
    }
    k
}

impl FromStr for Shard {
    type Err = FarmError;

    fn from_str(s: &str) -> Result<Shard, FarmError> {
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| FarmError::ShardSyntax(s.into()))?;
        let p = |v: &str| {
            v.trim()
                .parse::<usize>()
                .map_err(|_| FarmError::ShardSyntax(s.into()))
        };
        Shard::new(p(i)?, p(n)?)
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_unit_belongs_to_exactly_one_shard() {
        for total in [0, 1, 7, 8, 24, 100] {
            for count in [1, 2, 3, 8, 13, 150] {
                let mut seen = vec![0u32; total];
                for index in 0..count {
                    let s = Shard::new(index, count).unwrap();
                    let units = s.units(total);
                    assert!(units.windows(2).all(|w| w[0] < w[1]), "in order");
                    // Shares differ by at most one unit.
                    assert!(units.len().abs_diff(total / count) <= 1, "{total}/{count}");
                    for u in units {
                        assert!(s.owns(u, total));
                        seen[u] += 1;
                    }
                }
                assert!(
                    seen.iter().all(|&c| c == 1),
                    "{total} units, {count} shards"
                );
            }
        }
    }

    #[test]
    fn a_grid_of_tiles_is_spread_over_the_tasks_not_cut_into_columns() {
        // 8 columns x 4 rows, 8 tasks: each task gets tiles of at least 3 columns and 3 rows.
        for index in 0..8 {
            let units = Shard::new(index, 8).unwrap().units(32);
            assert_eq!(units.len(), 4);
            let cols: std::collections::BTreeSet<_> = units.iter().map(|u| u % 8).collect();
            let rows: std::collections::BTreeSet<_> = units.iter().map(|u| u / 8).collect();
            assert!(cols.len() >= 3 && rows.len() >= 3, "{units:?}");
        }
    }

    #[test]
    fn shards_parse_and_out_of_range_ones_are_refused() {
        assert_eq!(
            "3/8".parse::<Shard>().unwrap(),
            Shard { index: 3, count: 8 }
        );
        assert!(matches!(
            "8/8".parse::<Shard>(),
            Err(FarmError::ShardOutOfRange { index: 8, count: 8 })
        ));
        let e = "9/8".parse::<Shard>().unwrap_err().to_string();
        assert!(e.contains("out of range") && e.contains("0..8"), "{e}");
        assert!(matches!(
            "0/0".parse::<Shard>(),
            Err(FarmError::ShardCount {
                count: 0,
                max: MAX_SHARDS
            })
        ));
        for bad in ["3", "a/8", "3/", "-1/8", ""] {
            assert!(
                matches!(bad.parse::<Shard>(), Err(FarmError::ShardSyntax(_))),
                "{bad}"
            );
        }
    }

    #[test]
    fn slurm_array_variables_give_the_shard() {
        let env = |vars: &'static [(&'static str, &'static str)]| {
            move |k: &str| {
                vars.iter()
                    .find(|(n, _)| *n == k)
                    .map(|(_, v)| v.to_string())
            }
        };
        assert_eq!(Shard::from_vars(env(&[])).unwrap(), None);
        let s = Shard::from_vars(env(&[
            ("SLURM_ARRAY_TASK_ID", "5"),
            ("SLURM_ARRAY_TASK_COUNT", "8"),
            ("SLURM_ARRAY_TASK_MIN", "0"),
        ]));
        assert_eq!(s.unwrap(), Some(Shard { index: 5, count: 8 }));
        // --array=1-8 numbers tasks from 1.
        let s = Shard::from_vars(env(&[
            ("SLURM_ARRAY_TASK_ID", "8"),
            ("SLURM_ARRAY_TASK_COUNT", "8"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
        ]));
        assert_eq!(s.unwrap(), Some(Shard { index: 7, count: 8 }));
        assert!(matches!(
            Shard::from_vars(env(&[("SLURM_ARRAY_TASK_ID", "2")])),
            Err(FarmError::Env { .. })
        ));
        assert!(matches!(
            Shard::from_vars(env(&[
                ("SLURM_ARRAY_TASK_ID", "x"),
                ("SLURM_ARRAY_TASK_COUNT", "8")
            ])),
            Err(FarmError::Env { .. })
        ));
        assert!(matches!(
            Shard::from_vars(env(&[
                ("SLURM_ARRAY_TASK_ID", "9"),
                ("SLURM_ARRAY_TASK_COUNT", "8")
            ])),
            Err(FarmError::ShardOutOfRange { .. })
        ));
    }
}
