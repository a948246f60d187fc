//! Phase 3 of a frame, unification: bricks no ray visited for a while are unloaded.

use super::OctreeView;
use crate::evict::unify;

impl OctreeView {
    /// Phase 3: unloads every brick not visited since the last unification; returns how
    /// many. (A frame's own unification, [`OctreeView::step`], keeps bricks until they have gone
    /// unvisited [`IDLE_UNIFICATIONS`] times, unless memory runs short.)
    pub fn unify(&mut self) -> usize {
        self.unify_idle(1)
    }

    /// Unloads the bricks that have gone unvisited by `idle_limit` unifications in a row.
    pub(super) fn unify_idle(&mut self, idle_limit: u8) -> usize {
        let n = unify(&mut self.tree, self.cfg.keep_levels, idle_limit);
        if let Some((id, b)) = self.skip
            && (self.tree.nodes[id as usize].is_free()
                || self.tree.nodes[id as usize].depth != b.depth)
        {
            self.skip = None;
        }
        n
    }
}

/// A frame's unification unloads a brick once this many unifications in a row found it
/// unvisited (16 frames at the default period of 4; see [`crate::evict::unify`]).
pub const IDLE_UNIFICATIONS: u8 = 4;
