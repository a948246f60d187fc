//! The octree node as stored in the arena, and its flags.
//!
//! Nodes are addressed by `u32` ids into one `Vec` (no `Rc`/`Box` graph). The 8 children of a
//! node live in one block of 8 consecutive slots, so a node stores only the id of its first
//! child; the octant of a node is `id & 7`.
//!
//! Bytes per node (`size_of::<Node>() == 48`, checked by a test):
//!
//! | field        | bytes | why                                                           |
//! |--------------|-------|---------------------------------------------------------------|
//! | `nb[6]`      | 24    | neighbour links, one per face, optimised on the fly by rays   |
//! | `children`   | 4     | first child id (block of 8) or [`NONE`] for a leaf            |
//! | `parent`     | 4     | recombination, ascent during traversal and skip-node updates  |
//! | `brick`      | 4     | id of the brick representative (nearest brick ancestor)       |
//! | `colour`     | 4     | RGBA8; inner nodes hold the average of their full children   |
//! | `plane`      | 5     | a full leaf's surface plane ([`SurfacePlane`]), drawn when wide |
//! | `depth`      | 1     | level below the root (box size is `2^-depth` of the root)     |
//! | `flags`      | 1     | empty / requested / visited / free                            |
//! | `idle`       | 1     | unifications a brick has gone unvisited (unloaded at a limit) |
//!
//! The dissertation's Java node was 26 bytes of fields (plus JVM headers and one object per
//! child array); positions are not stored: boxes are recomputed exactly from the depth during
//! traversal (all coordinates are dyadic in root units).

use crate::plane::SurfacePlane;
use std::sync::atomic::{AtomicU8, AtomicU32, Ordering::Relaxed};

/// The null node id.
pub const NONE: u32 = u32::MAX;

/// Flag: the leaf holds no surface (meaningless on inner nodes).
pub const EMPTY: u8 = 1;
/// Flag: a ray asked for this full leaf to be subdivided this frame.
pub const REQUESTED: u8 = 2;
/// Flag (brick representatives): a ray passed through this brick since the last unification.
pub const VISITED: u8 = 4;
/// Flag: the slot is free (unallocated or unloaded).
pub const FREE: u8 = 8;

/// One octree node. Atomics are used only for what rays write while rendering (neighbour-link
/// optimisation, visited and requested flags); everything else changes between render phases.
#[repr(C)]
#[derive(Debug)]
pub struct Node {
    /// Neighbour link per face (`2 * axis + (positive ? 1 : 0)`): a node at the same or a
    /// coarser depth whose box contains this box shifted one box width through that face, or
    /// [`NONE`] at the root's boundary.
    pub nb: [AtomicU32; 6],
    /// Id of the first of the 8 children, or [`NONE`] for a leaf.
    pub children: u32,
    /// Parent id ([`NONE`] for the root).
    pub parent: u32,
    /// Brick representative: the nearest ancestor-or-self whose depth is a multiple of the
    /// brick period.
    pub brick: u32,
    /// RGBA8 colour of a full leaf, or the average of the children of an inner node.
    pub colour: u32,
    /// The surface plane a full leaf is drawn with while it is wider than a pixel (kept by
    /// inner nodes, which become leaves again when their brick is unloaded).
    pub plane: SurfacePlane,
    /// Depth below the root.
    pub depth: u8,
    /// [`EMPTY`], [`REQUESTED`], [`VISITED`], [`FREE`].
    pub flags: AtomicU8,
    /// Brick representatives: unifications in a row that found the brick unvisited (see
    /// [`crate::evict::unify`]); changed only between render phases.
    pub idle: u8,
}

impl Node {
    /// A free slot.
    pub fn free() -> Node {
        Node {
            nb: std::array::from_fn(|_| AtomicU32::new(NONE)),
            children: NONE,
            parent: NONE,
            brick: NONE,
            colour: 0,
            plane: SurfacePlane::NONE,
            depth: 0,
            flags: AtomicU8::new(FREE),
            idle: 0,
        }
    }

    /// True when the node has no children.
    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.children == NONE
    }

    /// Current flags.
    #[inline(always)]
    pub fn flags(&self) -> u8 {
        self.flags.load(Relaxed)
    }

    /// True for an empty leaf.
    #[inline(always)]
    pub fn is_empty(&self) -> bool {
        self.flags() & EMPTY != 0
    }

    /// True for a free slot.
    #[inline(always)]
    pub fn is_free(&self) -> bool {
        self.flags() & FREE != 0
    }

    /// Neighbour link through face `f`.
    #[inline(always)]
    pub fn link(&self, f: usize) -> u32 {
        self.nb[f].load(Relaxed)
    }

    /// Sets the neighbour link through face `f` (safe while rays run: any valid link will do).
    #[inline(always)]
    pub fn set_link(&self, f: usize, id: u32) {
        self.nb[f].store(id, Relaxed)
    }

    /// Sets flag bits.
    #[inline(always)]
    pub fn set_flags(&self, bits: u8) {
        self.flags.fetch_or(bits, Relaxed);
    }

    /// Clears flag bits.
    #[inline(always)]
    pub fn clear_flags(&self, bits: u8) {
        self.flags.fetch_and(!bits, Relaxed);
    }

    /// Sets `bits` and returns whether they were all clear before (first caller wins).
    ///
    /// A plain load first, the atomic read-modify-write only when the bits look clear: every
    /// ray that meets a voxel larger than its pixel asks for it, and with voxels tens of pixels
    /// wide thousands of rays a frame would otherwise write the same cache line from both
    /// cores (14 % of the Mandelbulb's ray casting went to that contended `lock cmpxchg`).
    #[inline(always)]
    pub fn claim(&self, bits: u8) -> bool {
        self.flags.load(Relaxed) & bits != bits && self.flags.fetch_or(bits, Relaxed) & bits == 0
    }
}

/// The face opposite `f`.
#[inline(always)]
pub fn opposite(f: usize) -> usize {
    f ^ 1
}

/// Packs linear RGB in [0, 1] into RGBA8 (sRGB-ish gamma 2.2 is applied at output, not here).
pub fn pack_rgb(c: [f64; 3]) -> u32 {
    let q = |v: f64| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u32;
    q(c[0]) | (q(c[1]) << 8) | (q(c[2]) << 16) | (255 << 24)
}

/// Unpacks RGBA8 into linear RGB in [0, 1].
pub fn unpack_rgb(c: u32) -> [f64; 3] {
    [
        (c & 255) as f64 / 255.0,
        ((c >> 8) & 255) as f64 / 255.0,
        ((c >> 16) & 255) as f64 / 255.0,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_is_48_bytes() {
        assert_eq!(std::mem::size_of::<Node>(), 48);
    }

    #[test]
    fn claim_is_first_wins_and_colours_round_trip() {
        let n = Node::free();
        assert!(n.claim(REQUESTED));
        assert!(!n.claim(REQUESTED));
        n.clear_flags(REQUESTED);
        assert!(n.claim(REQUESTED));
        let c = [0.2, 0.5, 1.0];
        let back = unpack_rgb(pack_rgb(c));
        for i in 0..3 {
            assert!((back[i] - c[i]).abs() < 0.003);
        }
        assert_eq!(opposite(0), 1);
        assert_eq!(opposite(5), 4);
    }
}
