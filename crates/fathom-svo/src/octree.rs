//! The octree arena: nodes in one `Vec` addressed by `u32`, children allocated in blocks of 8,
//! freed blocks recycled through a free list, and the exact box arithmetic of root units.
//!
//! Coordinates: the root is the cube `[0, 1)^3` in *root units*; world = `root_min +
//! u * root_size`. A node at depth `d` spans `2^-d`. Two box types (in [`crate::geometry`]):
//!
//! - [`Cell`]: the exact lattice position (integer coordinates at the box's depth, up to
//!   [`MAX_DEPTH`] = 100 levels, in `i128`). The structural code (linking, unification, link
//!   repair, the checker) works on cells, so it is exact at any depth and anywhere in the tree.
//! - [`BoxU`]: the box's minimum corner in f64 root units *relative to the [`Anchor`]*, a
//!   lattice point near the eye chosen each frame. The traversal and the evaluation of
//!   children work on these. Near the anchor every corner is a small dyadic number, exact in
//!   f64 however deep the box, so positions computed by halving (descent) or by stepping and
//!   snapping (neighbour traversal) agree bit for bit, as they did in absolute root units
//!   before (which ran out at depth 48: 2^-48 is 32 ulps of a coordinate in `[0.5, 1)`).
//!
//! Boxes are half-open: a point on a shared face belongs to the box on its positive side.

use crate::geometry::{BoxU, Cell, dim_at};
use crate::node::{EMPTY, FREE, NONE, Node};
use glam::DVec3;

/// Deepest level the octree will create. Box corners relative to the anchor are exact at any
/// depth; what bounds the depth is the scene's evaluation in double-double (106 bits of a root
/// coordinate: a box at depth 100 is 64 units of its last place) and the anchor's offsets
/// (below).
pub const MAX_DEPTH: u8 = 100;

/// Deepest anchor lattice: its coordinates and the per-depth offsets of coarser lattices are
/// then integers below 2^50 times `2^-depth`, exact in f64.
pub const MAX_ANCHOR_DEPTH: u8 = 50;

/// How many levels below the anchor boxes stay exact near the eye: a box at depth
/// `anchor + ANCHOR_SPAN` is `2^-ANCHOR_SPAN` of the anchor cell, 32 ulps of a local coordinate
/// in `[0.5, 1)` of it, the margin the root-unit boxes had at depth 48. Requests deeper than
/// this are refused (the anchor moves down with the zoom long before).
pub const ANCHOR_SPAN: u8 = 48;

/// The lattice point box corners are measured from: `cell * 2^-depth` in root units (it may
/// lie outside the root, as the Menger zoom's eye does). The octree view moves it with the eye
/// (`OctreeView::render`); with `depth` 0 and `cell` 0 local coordinates are root units.
#[derive(Clone, Debug, PartialEq)]
pub struct Anchor {
    /// Depth of the anchor's lattice, at most [`MAX_ANCHOR_DEPTH`].
    pub depth: u8,
    /// Lattice coordinates at `depth`.
    pub cell: [i128; 3],
    /// For `d < depth`: the local coordinate of the depth-`d` lattice plane at or below the
    /// anchor, per axis (a multiple of `2^-depth` in `(-2^-d, 0]`, exact). Zero at `d >= depth`,
    /// where the anchor itself lies on the lattice.
    off: Vec<[f64; 3]>,
    /// The root box in local coordinates (kept: rays entering the root ask for it).
    root: BoxU,
}

impl Default for Anchor {
    fn default() -> Self {
        Anchor::new(0, [0; 3])
    }
}

impl Anchor {
    /// The anchor at lattice point `cell` of depth `depth` (clamped to [`MAX_ANCHOR_DEPTH`]).
    pub fn new(depth: u8, cell: [i128; 3]) -> Anchor {
        let depth = depth.min(MAX_ANCHOR_DEPTH);
        let unit = dim_at(depth);
        let off = (0..depth)
            .map(|d| cell.map(|c| -(c.rem_euclid(1i128 << (depth - d)) as f64) * unit))
            .collect();
        let root = BoxU {
            min: cell.map(|c| -(c as f64) * unit),
            depth: 0,
        };
        Anchor {
            depth,
            cell,
            off,
            root,
        }
    }

    /// The anchor of depth `depth` at the lattice point at or below root-unit point `u`
    /// (given as an f64 pair `hi + lo`, so an eye known to double-double precision lands in
    /// the right cell).
    pub fn at(depth: u8, hi: [f64; 3], lo: [f64; 3]) -> Anchor {
        let depth = depth.min(MAX_ANCHOR_DEPTH);
        let scale = 1.0 / dim_at(depth);
        let cell = std::array::from_fn(|a| {
            // hi * 2^depth is exact (power of two); its floor plus the floor of the rest.
            let x = hi[a] * scale;
            let f = x.floor();
            let rest = (x - f) + lo[a] * scale;
            f as i128 + rest.floor() as i128
        });
        Anchor::new(depth, cell)
    }

    /// Root units of the anchor: `cell * 2^-depth`, as `hi + lo` (exact: at most 2^50 before
    /// scaling, so `lo` is 0 unless the anchor lies far outside the root).
    pub fn origin(&self) -> [(f64, f64); 3] {
        let unit = dim_at(self.depth);
        self.cell.map(|c| {
            let hi = c as f64;
            let lo = (c - hi as i128) as f64;
            (hi * unit, lo * unit)
        })
    }

    /// The root box in local coordinates.
    #[inline(always)]
    pub fn root_box(&self) -> BoxU {
        self.root
    }

    /// The box at depth `d <= b.depth` that contains `b`.
    #[inline(always)]
    pub fn snap(&self, b: &BoxU, d: u8) -> BoxU {
        if d >= self.depth {
            // The anchor lies on every lattice of depth `d >= self.depth`: local 0 is a corner.
            return b.snapped(d);
        }
        let s = dim_at(d);
        let inv = f64::from_bits((1023 + d as u64) << 52);
        let off = self.off[d as usize];
        let min = std::array::from_fn(|a| {
            // `b.min - off` exactly as hi + lo (it may need more than 53 bits when `b` is far
            // finer than `d`); the floor of the exact quotient, then back to local units.
            let (hi, lo) = two_sum(b.min[a], -off[a]);
            let y = hi * inv;
            let f = y.floor();
            let f = if f == y && lo < 0.0 { f - 1.0 } else { f };
            off[a] + f * s
        });
        BoxU { min, depth: d }
    }

    /// The parent box of `b`.
    #[inline(always)]
    pub fn parent(&self, b: &BoxU) -> BoxU {
        self.snap(b, b.depth - 1)
    }

    /// The exact lattice cell of a box computed by this anchor's arithmetic.
    pub fn cell_of(&self, b: &BoxU) -> Cell {
        let d = b.depth;
        let ijk = std::array::from_fn(|a| {
            if d >= self.depth {
                (self.cell[a] << (d - self.depth)) + (b.min[a] * (1.0 / dim_at(d))).round() as i128
            } else {
                let k = ((b.min[a] - self.off[d as usize][a]) * (1.0 / dim_at(d))).round() as i128;
                self.cell[a].div_euclid(1i128 << (self.depth - d)) + k
            }
        });
        Cell { ijk, depth: d }
    }

    /// The local box of a lattice cell (one rounding per coordinate: exact near the anchor).
    pub fn box_of(&self, c: &Cell) -> BoxU {
        let d = c.depth;
        let min = std::array::from_fn(|a| {
            if d >= self.depth {
                (c.ijk[a] - (self.cell[a] << (d - self.depth))) as f64 * dim_at(d)
            } else {
                ((c.ijk[a] << (self.depth - d)) - self.cell[a]) as f64 * dim_at(self.depth)
            }
        });
        BoxU { min, depth: d }
    }
}

/// `a + b` as an exact pair `(s, e)` with `s = fl(a + b)` (Knuth's two-sum).
#[inline(always)]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// Counts kept up to date by every structural change.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Allocated node slots (the root plus 8 per child block).
    pub nodes: usize,
    /// Bricks: inner nodes whose depth is a multiple of the brick period (the root included).
    pub bricks: usize,
}

/// The arena.
pub struct Octree {
    /// All slots; slots 1..8 are never used (the root has no siblings).
    pub nodes: Vec<Node>,
    free_blocks: Vec<u32>,
    pending_free: Vec<u32>,
    /// World position of the root's minimum corner.
    pub root_min: DVec3,
    /// World side of the root cube.
    pub root_size: f64,
    /// Bricks are created every `brick_period` levels.
    pub brick_period: u8,
    /// Most node slots the memory budget allows.
    pub max_nodes: usize,
    /// What [`BoxU`] coordinates are measured from (moved only between frames).
    pub anchor: Anchor,
    /// Full leaves wider than this many pixels are drawn with their surface plane
    /// ([`crate::plane`]); narrower ones, and all with `f64::INFINITY` (the default), as
    /// cubes.
    pub plane_px: f64,
    counts: Counts,
}

impl Octree {
    /// A tree of one root leaf spanning the cube `root_min + [0, root_size)^3`.
    pub fn new(root_min: DVec3, root_size: f64, brick_period: u8, max_nodes: usize) -> Octree {
        let mut nodes: Vec<Node> = (0..8).map(|_| Node::free()).collect();
        let root = &mut nodes[0];
        root.flags = std::sync::atomic::AtomicU8::new(0);
        root.brick = 0;
        root.colour = crate::node::pack_rgb([0.5; 3]);
        Octree {
            nodes,
            free_blocks: Vec::new(),
            pending_free: Vec::new(),
            root_min,
            root_size,
            brick_period: brick_period.max(1),
            max_nodes: max_nodes.max(9),
            anchor: Anchor::default(),
            plane_px: f64::INFINITY,
            counts: Counts {
                nodes: 1,
                bricks: 0,
            },
        }
    }

    /// Current counts.
    pub fn counts(&self) -> Counts {
        self.counts
    }

    /// Bytes held by the arena (capacity, not just live nodes).
    pub fn arena_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<Node>()
            + (self.free_blocks.capacity() + self.pending_free.capacity()) * 4
    }

    /// True when `depth` starts a brick.
    #[inline(always)]
    pub fn is_brick_depth(&self, depth: u8) -> bool {
        depth.is_multiple_of(self.brick_period)
    }

    /// World point to root units.
    #[inline(always)]
    pub fn to_u(&self, p: DVec3) -> [f64; 3] {
        let q = (p - self.root_min) / self.root_size;
        [q.x, q.y, q.z]
    }

    /// The root box in local coordinates.
    #[inline(always)]
    pub fn root_box(&self) -> BoxU {
        self.anchor.root_box()
    }

    /// Centre of a local box in world units *relative to the anchor's world position*
    /// (`root_min + origin * root_size`): small numbers with full f64 precision near the eye.
    pub fn centre_local(&self, b: &BoxU) -> DVec3 {
        let h = b.dim() * 0.5;
        DVec3::new(b.min[0] + h, b.min[1] + h, b.min[2] + h) * self.root_size
    }

    /// A point of local root units in world units relative to the anchor.
    pub fn local_world(&self, u: [f64; 3]) -> DVec3 {
        DVec3::from_array(u) * self.root_size
    }

    /// The deepest box the current anchor keeps exact near the eye.
    #[inline(always)]
    pub fn depth_limit(&self) -> u8 {
        (self.anchor.depth + ANCHOR_SPAN).min(MAX_DEPTH)
    }

    /// Whether the memory budget has no room for another block of 8 children: the one test
    /// allocation, the subdivision loops and the settling rounds all stop on.
    #[inline]
    pub fn is_full(&self) -> bool {
        self.counts.nodes + 8 > self.max_nodes
    }

    /// Allocates a block of 8 child slots, or `None` when the memory budget is exhausted.
    pub fn alloc_block(&mut self) -> Option<u32> {
        if self.is_full() {
            return None;
        }
        self.counts.nodes += 8;
        if let Some(b) = self.free_blocks.pop() {
            return Some(b);
        }
        let first = self.nodes.len() as u32;
        if self.nodes.len() == self.nodes.capacity() {
            // Grow by half, never past the budget.
            let want = (self.nodes.len() / 2)
                .max(4096)
                .min(self.max_nodes + 8 - self.nodes.len());
            self.nodes.reserve_exact(want.max(8));
        }
        self.nodes.extend((0..8).map(|_| Node::free()));
        Some(first)
    }

    /// Marks a block free now; its slots are reused only after [`Octree::commit_frees`], so
    /// ids held by this phase's work list can still be recognised as stale.
    pub fn release_block(&mut self, first: u32) {
        for i in first..first + 8 {
            let n = &mut self.nodes[i as usize];
            *n.flags.get_mut() = FREE;
            n.children = NONE;
            n.parent = NONE;
            for l in &mut n.nb {
                *l.get_mut() = NONE;
            }
        }
        self.counts.nodes -= 8;
        self.pending_free.push(first);
    }

    /// Moves released blocks onto the free list (end of a mutation phase).
    pub fn commit_frees(&mut self) {
        self.free_blocks.append(&mut self.pending_free);
    }

    /// Records that node `id` became an inner node (`true`) or a leaf again (`false`).
    pub(crate) fn note_inner(&mut self, id: u32, inner: bool) {
        let d = self.nodes[id as usize].depth;
        if self.is_brick_depth(d) {
            if inner {
                self.counts.bricks += 1;
            } else {
                self.counts.bricks -= 1;
            }
        }
    }

    /// Descends from the root to the leaf containing `p` (local units). `None` outside the root.
    pub fn locate(&self, p: [f64; 3]) -> Option<(u32, BoxU)> {
        let mut b = self.root_box();
        if !b.contains(p) {
            return None;
        }
        let mut id = 0u32;
        loop {
            let n = &self.nodes[id as usize];
            if n.is_leaf() {
                return Some((id, b));
            }
            let o = b.octant_of(p);
            id = n.children + o as u32;
            b = b.child(o);
        }
    }

    /// The lattice cell of node `id`, rebuilt from the octants on its path (exact at any
    /// depth; for the structural code, checks and tools).
    pub fn cell_of(&self, id: u32) -> Cell {
        let mut path = Vec::new();
        let mut i = id;
        while i != 0 {
            path.push((i & 7) as usize);
            i = self.nodes[i as usize].parent;
        }
        path.iter().rev().fold(Cell::ROOT, |c, &o| c.child(o))
    }

    /// True when `id` is a leaf without surface.
    pub fn is_empty_leaf(&self, id: u32) -> bool {
        let n = &self.nodes[id as usize];
        n.is_leaf() && n.flags() & EMPTY != 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_arithmetic_is_exact() {
        assert_eq!(dim_at(0), 1.0);
        assert_eq!(dim_at(3), 0.125);
        assert_eq!(dim_at(48), 2f64.powi(-48));
        let b = BoxU::ROOT.child(7).child(0).child(5);
        assert_eq!(b.min, [0.5 + 0.125, 0.5, 0.5 + 0.125]);
        let an = Anchor::default();
        assert_eq!(an.parent(&an.parent(&b)), BoxU::ROOT.child(7));
        let a = b.across(1);
        assert_eq!(a.min[0], b.min[0] + b.dim());
        assert_eq!(a.snapped(1), BoxU::ROOT.child(7));
        let (c7, cb) = (an.cell_of(&BoxU::ROOT.child(7)), an.cell_of(&b));
        assert!(c7.encloses(&cb));
        assert!(!cb.encloses(&c7));
        assert_eq!(cb, Cell::ROOT.child(7).child(0).child(5));
        assert_eq!(an.box_of(&cb), b);
        assert!(b.contains(b.min));
        assert!(!b.contains([b.min[0] + b.dim(), b.min[1], b.min[2]]));
    }

    /// A path of `depth` random octants from the root, as cells.
    fn random_path(depth: u8, seed: u64) -> Vec<Cell> {
        let mut x = seed;
        let mut c = Cell::ROOT;
        let mut out = vec![c];
        for _ in 0..depth {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            c = c.child((x >> 61) as usize);
            out.push(c);
        }
        out
    }

    #[test]
    fn boxes_relative_to_a_deep_anchor_are_exact_where_root_units_are_not() {
        // A path 96 levels deep (2^-96 of the root: far below an f64 ulp of a root coordinate),
        // with the anchor 40 levels above its end, at the corner of the cell the path passes.
        for seed in 1..20u64 {
            let path = random_path(96, seed);
            let leaf = path[96];
            let an = Anchor::new(50, path[50].ijk);
            assert_eq!(Anchor::new(56, path[56].ijk).depth, MAX_ANCHOR_DEPTH);
            // Descending in local f64 coordinates gives every cell's box exactly.
            let mut b = an.root_box();
            for (d, c) in path.iter().enumerate().skip(1) {
                b = b.child(
                    c.ijk
                        .iter()
                        .enumerate()
                        .fold(0, |o, (a, &i)| o | ((i & 1) as usize) << a),
                );
                assert_eq!(an.cell_of(&b), *c, "seed {seed} depth {d}");
                assert_eq!(an.box_of(c), b, "seed {seed} depth {d}");
            }
            // Snapping the leaf to every coarser depth (across more than 53 levels too) finds
            // the ancestor's box, the same as descending.
            let lb = an.box_of(&leaf);
            for d in (0..96u8).step_by(5) {
                assert_eq!(
                    an.cell_of(&an.snap(&lb, d)),
                    path[d as usize],
                    "seed {seed} snap to {d}"
                );
            }
            // Neighbours across faces, then snapped, are the lattice neighbours' ancestors.
            for f in 0..6 {
                let nb = an.box_of(&leaf.across(f));
                assert_eq!(an.cell_of(&nb), leaf.across(f));
                assert_eq!(an.cell_of(&an.snap(&nb, 7)), leaf.across(f).snapped(7));
            }
            // Root units could not even tell the leaf from its neighbour.
            let u = |c: &Cell| c.ijk[0] as f64 * dim_at(c.depth);
            assert_eq!(u(&leaf), u(&leaf.across(1)), "f64 root units resolve 2^-96");
        }
    }

    #[test]
    fn anchors_from_a_double_double_point_land_in_its_cell() {
        // The point 1 - 2^-70 (hi = 1, lo = -2^-70) lies in the last cell below 1 at depth 50.
        let an = Anchor::at(50, [1.0; 3], [-(2f64.powi(-70)); 3]);
        assert_eq!(an.cell, [(1i128 << 50) - 1; 3]);
        let o = an.origin();
        assert_eq!(o[0].0 + o[0].1, 1.0 - 2f64.powi(-50));
        // The root box's far face is at local 2^-50 along each axis.
        assert_eq!(an.root_box().min[0] + 1.0, 2f64.powi(-50));
    }

    #[test]
    fn blocks_are_recycled_only_after_commit_and_budget_holds() {
        let mut t = Octree::new(DVec3::splat(-2.0), 4.0, 3, 1 + 16);
        let a = t.alloc_block().unwrap();
        let b = t.alloc_block().unwrap();
        assert!(
            t.alloc_block().is_none(),
            "budget of 17 slots allows two blocks"
        );
        t.release_block(a);
        assert_eq!(t.counts().nodes, 9);
        let c = t.alloc_block().unwrap();
        assert_ne!(c, a, "released block must not be reused before commit");
        assert_ne!(c, b);
        t.release_block(c);
        t.commit_frees();
        let d = t.alloc_block().unwrap();
        assert!(d == a || d == c);
    }
}
