//! The skip node, the leaf that contains the eye and where rays start: kept up to date as the
//! eye moves (through the face it crossed, else by a descent from the root), and split while
//! the eye sits inside a coarse full voxel.

use super::OctreeView;
use crate::generate::{Outcome, apply, eval_children};
use crate::geometry::BoxU;
use crate::node::NONE;
use crate::shader::Probe;

impl OctreeView {
    /// The current skip node and its box.
    pub fn skip(&self) -> Option<(u32, BoxU)> {
        self.skip
    }

    /// Brings the skip node up to date for an eye at `o` (local units): stays if still valid,
    /// else follows the link through the face the eye crossed, else descends from the root.
    pub fn update_skip(&mut self, o: [f64; 3]) {
        let tree = &self.tree;
        if !tree.root_box().contains(o) {
            self.skip = None;
            return;
        }
        let descend = |mut id: u32, mut b: BoxU| {
            while !tree.nodes[id as usize].is_leaf() {
                let oc = b.octant_of(o);
                id = tree.nodes[id as usize].children + oc as u32;
                b = b.child(oc);
            }
            (id, b)
        };
        if let Some((id, b)) = self.skip
            && !tree.nodes[id as usize].is_free()
            && tree.nodes[id as usize].depth == b.depth
        {
            if b.contains(o) {
                self.skip = Some(descend(id, b));
                return;
            }
            // The face the eye left through: the axis of largest excursion.
            let s = b.dim();
            let mut best = (0.0, 0);
            for a in 0..3 {
                let ex = (b.min[a] - o[a]).max(o[a] - (b.min[a] + s));
                let f = 2 * a + (o[a] >= b.min[a] + s) as usize;
                if ex > best.0 {
                    best = (ex, f);
                }
            }
            let nb = tree.nodes[id as usize].link(best.1);
            if nb != NONE {
                let nbb = tree
                    .anchor
                    .snap(&b.across(best.1), tree.nodes[nb as usize].depth);
                if nbb.contains(o) {
                    self.skip = Some(descend(nb, nbb));
                    return;
                }
            }
        }
        self.skip = tree.locate(o);
    }

    /// The eye never sits inside the surface, but it can sit inside a coarse full voxel that
    /// the zoom has not refined yet: every ray would then stop at distance 0, nothing else
    /// would be visited, and unification would unload the whole view. Subdivide the eye's
    /// leaf (synchronously, it is one leaf per level) until it is empty or at the depth limit.
    pub(super) fn clear_eye(&mut self, o: [f64; 3]) {
        let mut ev = Probe::new();
        while let Some((id, b)) = self.skip {
            let n = &self.tree.nodes[id as usize];
            if n.is_empty() || !n.is_leaf() || b.depth >= self.tree.depth_limit() {
                return;
            }
            let r = eval_children(&self.shader, &self.tree, &mut ev, (id, b), 0.0);
            if apply(&mut self.tree, &r) == Outcome::NoMemory {
                return;
            }
            self.tree.commit_frees();
            self.skip = self.tree.locate(o);
        }
    }
}
