//! The link-integrity checker: walks the whole tree and verifies every structural invariant
//! the traversal relies on. Used by the tests after subdivision, recombination and
//! unification, and by the stress test every frame.

use crate::geometry::Cell;
use crate::node::{EMPTY, NONE};
use crate::octree::Octree;

/// Checks the tree; returns the first problem found.
///
/// Invariants: parent/child consistency; depths; brick representatives (nearest ancestor at a
/// brick depth); no live node is flagged free and no reachable slot is free; every neighbour
/// link is `NONE` exactly at the root's boundary, else names a live node no deeper than its
/// owner whose box contains the owner's box shifted through that face; no inner node has 8
/// empty leaf children (recombination); the node count matches the reachable nodes.
pub fn check(tree: &Octree) -> Result<(), String> {
    let nodes = &tree.nodes;
    let mut boxes: Vec<Option<Cell>> = vec![None; nodes.len()];
    let mut stack = vec![(0u32, Cell::ROOT)];
    let mut live = 0usize;
    let mut bricks = 0usize;
    while let Some((id, b)) = stack.pop() {
        let n = &nodes[id as usize];
        live += 1;
        if n.is_free() {
            return Err(format!("node {id} is reachable but flagged free"));
        }
        if n.depth != b.depth {
            return Err(format!(
                "node {id} has depth {} but sits at {}",
                n.depth, b.depth
            ));
        }
        let want_brick = if tree.is_brick_depth(b.depth) {
            id
        } else {
            nodes[n.parent as usize].brick
        };
        if n.brick != want_brick {
            return Err(format!(
                "node {id} names brick {} instead of {want_brick}",
                n.brick
            ));
        }
        boxes[id as usize] = Some(b);
        if n.children != NONE {
            if !n.children.is_multiple_of(8) || n.children == 0 {
                return Err(format!(
                    "node {id} has a misaligned child block {}",
                    n.children
                ));
            }
            if n.flags() & EMPTY != 0 {
                return Err(format!("inner node {id} is flagged empty"));
            }
            if tree.is_brick_depth(b.depth) {
                bricks += 1;
            }
            let mut all_empty = true;
            for o in 0..8 {
                let c = n.children + o;
                let cn = &nodes[c as usize];
                if cn.parent != id {
                    return Err(format!("child {c} of {id} names parent {}", cn.parent));
                }
                all_empty &= cn.is_leaf() && cn.is_empty();
                stack.push((c, b.child(o as usize)));
            }
            if all_empty {
                return Err(format!("inner node {id} has 8 empty leaf children"));
            }
        }
    }
    if live != tree.counts().nodes {
        return Err(format!(
            "{live} nodes reachable but the arena counts {}",
            tree.counts().nodes
        ));
    }
    if bricks != tree.counts().bricks {
        return Err(format!(
            "{bricks} bricks found but {} counted",
            tree.counts().bricks
        ));
    }
    for (id, b) in boxes.iter().enumerate() {
        let Some(b) = b else { continue };
        for f in 0..6 {
            let l = nodes[id].link(f);
            let shifted = b.across(f);
            let outside = !shifted.in_root();
            if l == NONE {
                if !outside {
                    return Err(format!(
                        "node {id} has no link through face {f} inside the root"
                    ));
                }
                continue;
            }
            if outside {
                return Err(format!(
                    "node {id} links through the root boundary (face {f})"
                ));
            }
            let Some(lb) = boxes.get(l as usize).copied().flatten() else {
                return Err(format!(
                    "node {id} face {f} links to dead node {l} (dangling)"
                ));
            };
            if lb.depth > b.depth || !lb.encloses(&shifted) {
                return Err(format!(
                    "node {id} (depth {}) face {f} links to {l} (depth {}) which does not hold the adjacent box",
                    b.depth, lb.depth
                ));
            }
        }
    }
    Ok(())
}
