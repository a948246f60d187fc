//! Bounded memory: bricks, visited flags and the not-recently-used unification.
//!
//! A brick is the subtree under a node whose depth is a multiple of the brick period `k`, so
//! bricks keep being created as the zoom deepens and the smallest ones never hold more than
//! `8^k` nodes. Every node names its brick representative; a ray marks the bricks of the
//! leaves it passes through (walking up the chain of enclosing bricks until one is already
//! marked). Every few frames, [`unify`] turns each brick that has gone unvisited long enough
//! (a few unifications in a row; one under memory pressure) into a single full leaf holding its
//! average colour, frees its nodes, and repairs the neighbour links that pointed
//! into them: those can only come from smaller nodes touching the brick's faces, so a walk
//! over the six face-adjacent regions finds them all. Freed child blocks go to the arena's
//! free list.

use crate::geometry::Cell;
use crate::node::{EMPTY, FREE, NONE, VISITED, opposite};
use crate::octree::Octree;

/// Marks the bricks enclosing node `id` as visited (rays call this; atomics, no locks). The
/// walk stops at the first brick already marked: a marked brick always has every enclosing
/// brick marked (new children are marked with their ancestors in `generate::apply`, and
/// [`unify`] clears every mark, leaf bricks included).
#[inline]
pub fn mark_visited(tree: &Octree, id: u32) {
    let nodes = &tree.nodes;
    let mut b = nodes[id as usize].brick;
    while b != NONE {
        let n = &nodes[b as usize];
        if n.flags() & VISITED != 0 {
            break;
        }
        n.set_flags(VISITED);
        let p = n.parent;
        if p == NONE {
            break;
        }
        b = nodes[p as usize].brick;
    }
}

/// Frees every descendant of `r` (box `rb`), repairing links into them so they point at `r`;
/// `r` becomes a leaf (its flags are left for the caller to set).
pub fn free_children(tree: &mut Octree, r: u32, rb: Cell) {
    let first = tree.nodes[r as usize].children;
    if first == NONE {
        return;
    }
    // 1. Collect the blocks of the subtree and mark their slots free.
    let mut blocks = Vec::new();
    let mut stack = vec![r];
    while let Some(x) = stack.pop() {
        let c = tree.nodes[x as usize].children;
        if c == NONE {
            continue;
        }
        tree.note_inner(x, false);
        blocks.push(c);
        for i in c..c + 8 {
            tree.nodes[i as usize].set_flags(FREE);
            stack.push(i);
        }
    }
    tree.nodes[r as usize].children = NONE;
    // 2. Repair links from outside that pointed into the freed nodes.
    let rdepth = rb.depth;
    for g in 0..6 {
        let start = tree.nodes[r as usize].link(g);
        if start == NONE {
            continue;
        }
        let a = rb.across(g);
        let axis = g >> 1;
        let sb = a.snapped(tree.nodes[start as usize].depth);
        let mut st = vec![(start, sb)];
        while let Some((y, yb)) = st.pop() {
            let n = &tree.nodes[y as usize];
            if yb.depth > rdepth {
                let l = n.link(opposite(g));
                if l != NONE && tree.nodes[l as usize].is_free() {
                    n.set_link(opposite(g), r);
                }
            }
            if n.children == NONE {
                continue;
            }
            for o in 0..8 {
                let cb = yb.child(o);
                // Compared as lattice coordinates at the finer of the two depths (exact).
                let d = cb.depth.max(a.depth);
                let touches = if g & 1 == 1 {
                    cb.span_at(axis, d).0 == a.span_at(axis, d).0
                } else {
                    cb.span_at(axis, d).1 == rb.span_at(axis, d).0
                };
                let overlaps = (0..3).filter(|&b| b != axis).all(|b| {
                    let (c, s) = (cb.span_at(b, d), a.span_at(b, d));
                    c.0 < s.1 && c.1 > s.0
                });
                if touches && overlaps {
                    st.push((n.children + o as u32, cb));
                }
            }
        }
    }
    // 3. Hand the blocks back (reused after this phase).
    for b in blocks {
        tree.release_block(b);
    }
}

/// Unloads every brick that has gone unvisited by `idle_limit` calls in a row, this one
/// included (1: not visited since the last call), except those shallower than `keep_levels`:
/// each becomes one full leaf with its average colour. Clears the visited flags of the bricks
/// kept. Returns how many bricks were unified.
///
/// Why not always 1: a zoom uncovers, through the holes of the near geometry, background it
/// saw a few frames before; unloaded at once, that background came back at the coarsest kept
/// level, voxels hundreds of pixels wide (Menger to 1e15, 300 frames, 640x480: median largest
/// visible voxel 70-73 px when unloading after 4 frames unseen, 31-33 px after 16).
pub fn unify(tree: &mut Octree, keep_levels: u8, idle_limit: u8) -> usize {
    let mut unified = 0;
    let mut stack = vec![(0u32, Cell::ROOT)];
    while let Some((x, xb)) = stack.pop() {
        let (first, flags) = {
            let n = &tree.nodes[x as usize];
            (n.children, n.flags())
        };
        if first == NONE {
            continue;
        }
        if tree.is_brick_depth(xb.depth) {
            let n = &mut tree.nodes[x as usize];
            n.idle = if flags & VISITED == 0 {
                n.idle.saturating_add(1)
            } else {
                0
            };
            if xb.depth >= keep_levels && n.idle >= idle_limit.max(1) {
                n.idle = 0;
                free_children(tree, x, xb);
                tree.nodes[x as usize].clear_flags(EMPTY);
                unified += 1;
                continue;
            }
            tree.nodes[x as usize].clear_flags(VISITED);
        }
        // Leaves at a brick depth are bricks too: clear their marks, or a stale mark would
        // stop `mark_visited`'s upward walk once the leaf is split, and the bricks above it
        // would go unmarked and be unloaded while in view.
        let leaf_bricks = tree.is_brick_depth(xb.depth + 1);
        for o in 0..8 {
            let c = &tree.nodes[(first + o) as usize];
            if c.children != NONE {
                stack.push((first + o, xb.child(o as usize)));
            } else if leaf_bricks {
                c.clear_flags(VISITED);
            }
        }
    }
    tree.commit_frees();
    unified
}
