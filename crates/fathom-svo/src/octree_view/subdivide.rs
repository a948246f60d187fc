//! Phase 2 of a frame, subdivision: the requested leaves split in order (largest on screen
//! first, nearer the centre counted larger) within a time budget, their children evaluated
//! in parallel and linked in on one thread.

use super::OctreeView;
use crate::generate::{Children, Outcome, apply, eval_children};
use crate::node::REQUESTED;
use crate::request_order::RequestQueue;
use crate::shader::Probe;
use crate::traverse::Request;
use rayon::prelude::*;
use std::time::Instant;

impl OctreeView {
    /// Phase 2: subdivides requested leaves in [`RequestQueue`] order (largest on screen
    /// first, nearer the centre counted larger) within the time budget. Returns
    /// (split, emptied, no-memory).
    pub fn subdivide(&mut self, reqs: Vec<Request>, budget_ms: f64) -> [u64; 3] {
        self.subdivide_until(reqs, budget_ms, &|| false)
    }

    /// [`OctreeView::subdivide`], stopping early at the first batch after `stop` returns true
    /// (a window's view moved on: a still view's long budget gives way within a batch).
    pub fn subdivide_until(
        &mut self,
        reqs: Vec<Request>,
        budget_ms: f64,
        stop: &dyn Fn() -> bool,
    ) -> [u64; 3] {
        let floor = self.cfg.min_subdivisions;
        self.subdivide_within(reqs, budget_ms, floor, stop)
    }

    /// [`OctreeView::subdivide_until`] with `floor` for the subdivisions done whatever the
    /// time ([`OctreeViewConfig::min_subdivisions`]).
    pub(super) fn subdivide_within(
        &mut self,
        reqs: Vec<Request>,
        budget_ms: f64,
        floor: usize,
        stop: &dyn Fn() -> bool,
    ) -> [u64; 3] {
        let t0 = Instant::now();
        let fovea = self.fovea;
        let mut reqs = self.pool.install(|| RequestQueue::new(reqs, &fovea));
        let mut out = [0u64; 3];
        let mut next = 0;

        // The floor is a cost, not a count: a deep frame's subdivisions evaluate in
        // double-double, ~5x the f64 time, and a floor of 256 of them would take ~80 ms.
        let weight = if self.tree.anchor.depth > 0 {
            DEEP_COST
        } else {
            1
        };
        // Batches of 64 f64 subdivisions' worth per thread, so the time check comes as often.
        let batch = (64 / weight).max(1) * self.cfg.threads.max(1);
        let mut done_min = 0;
        // Wall time one subdivision took in the batches so far (all threads, linking included).
        let mut per_sub_ms: Option<f64> = None;
        while next < reqs.len() {
            let elapsed = t0.elapsed().as_secs_f64() * 1e3;
            if (done_min >= floor && elapsed >= budget_ms) || stop() {
                break;
            }
            if self.tree.is_full() {
                break;
            }
            // Below the floor, no more than it still needs: a whole batch of double-double
            // subdivisions past it (72 where 52 reach it) took deep frames to 15-19 ms.
            // Past it, no more than the time left is expected to hold (at least one per
            // thread): whole batches ran a Menger zoom's 12 ms budget to 14 ms a frame.
            let size = if done_min < floor {
                batch.min((floor - done_min).div_ceil(weight))
            } else if let Some(c) = per_sub_ms {
                let fit = ((budget_ms - elapsed) / c).floor();
                if fit < 1.0 {
                    break;
                }
                batch.min((fit as usize).max(self.cfg.threads.max(1)))
            } else {
                batch
            };
            let end = (next + size).min(reqs.len());
            // Taken before the batch's clock starts: a sort past the first selection is not
            // a split's time.
            let chunk = self.pool.install(|| reqs.take(next, end));
            let tb = Instant::now();
            let tree = &self.tree;
            let sh = &self.shader;
            let lod = self.lod;
            let results: Vec<Children> = self.pool.install(|| {
                chunk
                    .par_iter()
                    .map_init(Probe::new, |ev, r| {
                        eval_children(sh, tree, ev, (r.id, r.b), r.t * lod)
                    })
                    .collect()
            });
            for r in &results {
                match apply(&mut self.tree, r) {
                    Outcome::Split => out[0] += 1,
                    Outcome::Emptied => out[1] += 1,
                    Outcome::NoMemory => out[2] += 1,
                    Outcome::Stale => {}
                }
            }
            done_min += chunk.len() * weight;
            per_sub_ms = Some(tb.elapsed().as_secs_f64() * 1e3 / chunk.len() as f64);
            next = end;
        }
        for r in reqs.from(next) {
            self.tree.nodes[r.id as usize].clear_flags(REQUESTED);
        }
        if next < reqs.len() && self.tree.is_full() {
            out[2] += (reqs.len() - next) as u64;
        }
        self.tree.commit_frees();
        out
    }

    /// Clears the requested flags of requests that will not be processed (after a render
    /// whose requests are dropped).
    pub fn release_requests(&self, reqs: &[Request]) {
        for r in reqs {
            self.tree.nodes[r.id as usize].clear_flags(REQUESTED);
        }
    }
}

/// What one subdivision on a deep frame (double-double evaluation) counts towards
/// [`OctreeViewConfig::min_subdivisions`](crate::OctreeViewConfig::min_subdivisions): `fathom bench
/// eval` measures double-double evaluation at 3.9-6.5x f64 for the fractal presets (5.8 Menger, 5.5
/// Mandelbulb).
pub const DEEP_COST: usize = 5;
