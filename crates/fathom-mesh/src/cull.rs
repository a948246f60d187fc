//! Empty-space skipping: an octree over the bricks, descended one z-layer at a time, keeping a
//! node only where the distance bound says the surface may cross it.
//!
//! A node is dropped when `|d(centre)| > margin * r`, `r` its half-diagonal: with a true
//! distance bound no surface point is then within the node. A node that touches the grid's
//! faces is kept whenever it may be inside (`d(centre) <= margin * r`), since the mesh closes
//! an object off at the bounds there. Only the survivors' children are tested, so the work
//! follows the surface, not the N^3 volume. The descent keeps, per level, the survivors whose
//! z-slab holds the current layer, and refreshes a level only when the layer enters a new slab
//! of it, so each node is tested once.

use crate::grid::{BRICK, Grid};
use fathom_core::{Evaluator, Tape, V3};
use rayon::prelude::*;

/// The layer-by-layer octree descent.
pub struct Culler<'a> {
    tape: &'a Tape,
    grid: Grid,
    margin: f64,
    /// Levels above the bricks: the root covers `2^top` bricks per side.
    top: u32,
    /// Survivors per level (index = level) for the current layer's slabs.
    levels: Vec<Vec<[u32; 3]>>,
    /// Nodes tested so far.
    pub tested: u64,
    /// Skip the test (keep every node): the dense reference.
    keep_all: bool,
}

impl<'a> Culler<'a> {
    pub fn new(tape: &'a Tape, grid: Grid, margin: f64, keep_all: bool) -> Self {
        let b = grid.bricks();
        let top = b
            .iter()
            .map(|&n| n.next_power_of_two().trailing_zeros())
            .max()
            .unwrap();
        Culler {
            tape,
            grid,
            margin,
            top,
            levels: vec![Vec::new(); top as usize + 1],
            tested: 0,
            keep_all,
        }
    }

    /// Whether the node (level, x, y, z) may hold surface.
    fn keep(&self, ev: &mut Evaluator<f64>, level: u32, n: [u32; 3]) -> bool {
        let span = (BRICK as i64) << level;
        let lo = n.map(|v| v as i64 * span);
        if (0..3).any(|a| lo[a] >= self.grid.cells[a] as i64) {
            return false;
        }
        if self.keep_all {
            return true;
        }
        let hi = lo.map(|v| v + span);
        let (plo, phi) = (self.grid.corner(lo), self.grid.corner(hi));
        let c = (plo + phi) * 0.5;
        let r = (phi - plo).length() * 0.5 * self.margin;
        let d = ev.distance(self.tape, V3::new(c.x, c.y, c.z));
        if d > r {
            return false;
        }
        let touches_face = (0..3).any(|a| lo[a] <= 0 || hi[a] >= self.grid.cells[a] as i64);
        d >= -r || touches_face
    }

    /// The active bricks of layer `z` (layers in increasing order), sorted by (y, x).
    pub fn layer(&mut self, z: u32) -> Vec<[u32; 3]> {
        self.descend(z, 0)
    }

    /// Descends to `stop` for the slab of layer `z`; returns the survivors at `stop`.
    pub fn descend(&mut self, z: u32, stop: u32) -> Vec<[u32; 3]> {
        for level in (stop..=self.top).rev() {
            if !z.is_multiple_of(1 << level) {
                continue; // still inside this level's slab: its survivors stand
            }
            let zl = z >> level;
            let candidates: Vec<[u32; 3]> = if level == self.top {
                vec![[0, 0, zl]]
            } else {
                self.levels[level as usize + 1]
                    .iter()
                    .flat_map(|p| {
                        [[0, 0], [1, 0], [0, 1], [1, 1]]
                            .map(|[dx, dy]| [2 * p[0] + dx, 2 * p[1] + dy, zl])
                    })
                    .collect()
            };
            self.tested += candidates.len() as u64;
            let this = &*self;
            let mut kept: Vec<[u32; 3]> = candidates
                .par_chunks(64)
                .flat_map_iter(|chunk| {
                    let mut ev = Evaluator::<f64>::new();
                    chunk
                        .iter()
                        .filter(|&&n| this.keep(&mut ev, level, n))
                        .copied()
                        .collect::<Vec<_>>()
                })
                .collect();
            kept.sort_unstable_by_key(|n| (n[1], n[0]));
            self.levels[level as usize] = kept;
        }
        self.levels[stop as usize].clone()
    }

    /// Levels above the bricks.
    pub fn top(&self) -> u32 {
        self.top
    }
}
