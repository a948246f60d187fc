//! The octree arena: nodes in one `Vec` addressed by `u32`, children allocated in blocks of 8,
//! freed blocks recycled through a free list, and the exact box arithmetic of root units.
//!
//! Coordinates: the root is the cube `[0, 1)^3` in *root units*; world = `root_min +
//! u * root_size`. A node at depth `d` spans `2^-d`, and every box corner is a dyadic number,
//! so box positions computed by halving (descent) or by stepping and snapping (neighbour
//! traversal) are exact and agree bit for bit. Boxes are half-open: a point on a shared face
//! belongs to the box on its positive side.

use crate::node::{EMPTY, FREE, NONE, Node};
use glam::DVec3;

/// Deepest level the octree will create. A box at depth 48 is `2^-48` of the root, 32 ulps of
/// a coordinate in `[0.5, 1)`: below that, ray positions are too coarse to tell voxels apart.
pub const MAX_DEPTH: u8 = 48;

/// A box in root units: its minimum corner and depth (side `2^-depth`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxU {
    /// Minimum corner.
    pub min: [f64; 3],
    /// Depth below the root.
    pub depth: u8,
}

impl BoxU {
    /// The root box.
    pub const ROOT: BoxU = BoxU {
        min: [0.0; 3],
        depth: 0,
    };

    /// Side length `2^-depth`.
    #[inline(always)]
    pub fn dim(&self) -> f64 {
        dim_at(self.depth)
    }

    /// Box of child `octant` (bit 0: +x half, bit 1: +y, bit 2: +z).
    #[inline(always)]
    pub fn child(&self, octant: usize) -> BoxU {
        let h = dim_at(self.depth + 1);
        let mut min = self.min;
        for (a, m) in min.iter_mut().enumerate() {
            if octant >> a & 1 == 1 {
                *m += h;
            }
        }
        BoxU {
            min,
            depth: self.depth + 1,
        }
    }

    /// The parent box (snap the corner onto the coarser grid).
    #[inline(always)]
    pub fn parent(&self) -> BoxU {
        self.snapped(self.depth - 1)
    }

    /// The box at depth `d <= self.depth` that contains this one.
    #[inline(always)]
    pub fn snapped(&self, d: u8) -> BoxU {
        let s = dim_at(d);
        // Scaling by a power of two is exact, so this equals `(m / s).floor() * s`.
        let inv = f64::from_bits((1023 + d as u64) << 52);
        BoxU {
            min: self.min.map(|m| (m * inv).floor() * s),
            depth: d,
        }
    }

    /// Half-open containment of a point.
    #[inline(always)]
    pub fn contains(&self, p: [f64; 3]) -> bool {
        let s = self.dim();
        (0..3).all(|a| p[a] >= self.min[a] && p[a] < self.min[a] + s)
    }

    /// Octant of the child containing `p` (assumes the box contains `p`).
    #[inline(always)]
    pub fn octant_of(&self, p: [f64; 3]) -> usize {
        let h = dim_at(self.depth + 1);
        let mut o = 0;
        for a in 0..3 {
            if p[a] >= self.min[a] + h {
                o |= 1 << a;
            }
        }
        o
    }

    /// The same-size box across face `f`.
    #[inline(always)]
    pub fn across(&self, f: usize) -> BoxU {
        let a = f >> 1;
        let delta = if f & 1 == 1 { self.dim() } else { -self.dim() };
        let c = |i: usize| {
            if i == a {
                self.min[i] + delta
            } else {
                self.min[i]
            }
        };
        BoxU {
            min: [c(0), c(1), c(2)],
            depth: self.depth,
        }
    }

    /// True when `other` lies inside this box.
    pub fn encloses(&self, other: &BoxU) -> bool {
        other.depth >= self.depth
            && (0..3).all(|a| {
                other.min[a] >= self.min[a]
                    && other.min[a] + other.dim() <= self.min[a] + self.dim()
            })
    }
}

/// Side of a box at depth `d`: `2^-d` (exact).
#[inline(always)]
pub fn dim_at(d: u8) -> f64 {
    f64::from_bits((1023 - d as u64) << 52)
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

    /// World centre of a box.
    pub fn centre_world(&self, b: &BoxU) -> DVec3 {
        let h = b.dim() * 0.5;
        self.root_min + DVec3::new(b.min[0] + h, b.min[1] + h, b.min[2] + h) * self.root_size
    }

    /// Allocates a block of 8 child slots, or `None` when the memory budget is exhausted.
    pub fn alloc_block(&mut self) -> Option<u32> {
        if self.counts.nodes + 8 > self.max_nodes {
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

    /// Descends from the root to the leaf containing `p` (root units). `None` outside the root.
    pub fn locate(&self, p: [f64; 3]) -> Option<(u32, BoxU)> {
        let mut b = BoxU::ROOT;
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

    /// The box of node `id`, rebuilt from the octants on its path (for checks and tools).
    pub fn box_of(&self, id: u32) -> BoxU {
        let mut path = Vec::new();
        let mut i = id;
        while i != 0 {
            path.push((i & 7) as usize);
            i = self.nodes[i as usize].parent;
        }
        let mut b = BoxU::ROOT;
        for &o in path.iter().rev() {
            b = b.child(o);
        }
        b
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
        assert_eq!(b.parent().parent(), BoxU::ROOT.child(7));
        let a = b.across(1);
        assert_eq!(a.min[0], b.min[0] + b.dim());
        assert_eq!(a.snapped(1), BoxU::ROOT.child(7));
        assert!(BoxU::ROOT.child(7).encloses(&b));
        assert!(!b.encloses(&BoxU::ROOT.child(7)));
        assert!(b.contains(b.min));
        assert!(!b.contains([b.min[0] + b.dim(), b.min[1], b.min[2]]));
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
