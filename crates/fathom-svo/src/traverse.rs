//! Ray casting through the octree: scale-independent neighbour traversal with a skip node and
//! on-the-fly link optimisation, and the kd-restart baseline.
//!
//! Both walk the same sequence of leaves and return bit-identical results on the same tree:
//! - a ray is `o + t d` in local root units (relative to the tree's [`Anchor`](crate::octree::Anchor),
//!   a lattice point near the eye; `d` unit length, so `t` is a distance in root units);
//! - the leaf at a point is the one whose half-open box contains it; boxes are exact dyadics
//!   near the anchor at any depth;
//! - leaving an empty leaf, `t` becomes the exit distance and the point is put exactly on the
//!   far side of the exit face (the face coordinate, or the float just below it);
//! - implicit LOD: the ray stops at the topmost inner node on the root-to-leaf path of the
//!   point whose side is below `t * lod`, returning that node's average colour.
//!
//! kd-restart finds each leaf by descending from the root. Neighbour traversal steps through
//! the exit face's link (a same-or-coarser node), climbs while the point is outside the box or
//! the parent already satisfies the LOD test (corner cases and LOD agreement), then descends.
//! The first leaf is the skip node (the leaf containing the eye), so a ray never descends from
//! the root when the eye is inside it; with the eye outside the root, the first leaf is found
//! from the previous ray's entry node (see [`cast_neighbour`]). When a link pointed to a
//! coarser node, the deepest node of the descent no deeper than the link's owner replaces it
//! (an atomic store: any valid link is correct, a better one only saves steps).

use crate::evict::mark_visited;
use crate::geometry::{BoxU, Ray, dim_at, enter_root, exit};
use crate::node::{NONE, REQUESTED};
use crate::octree::Octree;

/// Most node steps one ray may take before it is declared a miss (a guard, never reached on a
/// consistent tree).
pub const MAX_STEPS: u32 = 1 << 16;

/// What a ray found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance in root units where the ray stopped at the node (`f64::INFINITY` for a miss):
    /// the node's size on screen is its side over this.
    pub t: f64,
    /// Distance the pixel is drawn at, its depth: `t`, or beyond it where the ray reaches
    /// the leaf's surface plane ([`crate::plane::SurfacePlane::depth`]).
    pub drawn: f64,
    /// RGBA8 colour of the node hit (0 for a miss).
    pub colour: u32,
    /// Node hit, or [`NONE`].
    pub node: u32,
    /// Nodes stepped through (descents, ascents and neighbour steps, plus one).
    pub steps: u32,
    /// Depth of the node hit (its side is [`dim_at`] of it; 0 for a miss), so the caller
    /// need not load the node again.
    pub depth: u8,
}

impl Hit {
    /// A miss after `steps` (with 0, also a lattice slot before its ray is cast).
    pub(crate) fn miss(steps: u32) -> Hit {
        Hit {
            t: f64::INFINITY,
            drawn: f64::INFINITY,
            colour: 0,
            node: NONE,
            steps,
            depth: 0,
        }
    }

    /// True when the ray hit a voxel.
    pub fn is_hit(&self) -> bool {
        self.node != NONE
    }
}

/// A full leaf a ray found larger than its pixel footprint.
#[derive(Clone, Copy, Debug)]
pub struct Request {
    /// The leaf.
    pub id: u32,
    /// Its box.
    pub b: BoxU,
    /// Distance (root units) at which the ray that asked reached it: `b.dim() / t` is its
    /// angular size on screen, the order in which requests are served.
    pub t: f64,
}

impl Request {
    /// Angular size on screen (radians, small-angle): side over distance; infinite at `t = 0`.
    pub fn footprint(&self) -> f64 {
        self.b.dim() / self.t
    }
}

/// Where a ray starts: the leaf containing the eye and its box.
pub type Start = Option<(u32, BoxU)>;

/// The leaf (or LOD-terminating inner node) handling shared by both traversals. Returns the
/// hit when the ray stops here: a full leaf wider than the ray's pixel is met where the ray
/// meets its solid part ([`crate::plane::SurfacePlane::meet`]), and passed through when it
/// misses it (it still asks for the leaf's subdivision); below the planes' threshold it stops
/// at the cube, drawn at the depth of its plane ([`crate::plane::SurfacePlane::depth`]).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn stop_here(
    tree: &Octree,
    r: &Ray,
    id: u32,
    b: &BoxU,
    t: f64,
    lod: f64,
    steps: u32,
    last_brick: &mut u32,
    reqs: &mut Vec<Request>,
) -> Option<Hit> {
    let n = &tree.nodes[id as usize];
    // Leaves of one brick share its whole chain of enclosing bricks: mark it once per change
    // of brick along the ray, not at every leaf.
    if n.brick != *last_brick {
        *last_brick = n.brick;
        mark_visited(tree, id);
    }
    if n.is_empty() {
        return None;
    }
    let (mut t_hit, mut drawn) = (t, t);
    if b.dim() > t * lod {
        if b.depth < tree.depth_limit() && n.claim(REQUESTED) {
            reqs.push(Request { id, b: *b, t });
        }
        if n.plane.is_some() {
            if b.dim() > t * lod * tree.plane_px {
                t_hit = n.plane.meet(r, b, t)?;
                drawn = t_hit;
            } else {
                drawn = n.plane.depth(r, b, t);
            }
        }
    }
    Some(Hit {
        t: t_hit,
        drawn,
        colour: n.colour,
        node: id,
        steps,
        depth: b.depth,
    })
}

/// Neighbour traversal from the skip node (`start`, the leaf containing the eye). When the
/// eye is outside the root (`start` is `None`), the ray enters through the root's boundary and
/// its first leaf is found by climbing from `entry` (the node where the previous ray of this
/// worker entered, updated here) to the first node containing the entry point, then
/// descending: neighbouring rays enter through the same or nearby leaves, so this costs a step
/// or two instead of a descent from the root. The leaf found is the same either way.
pub fn cast_neighbour(
    tree: &Octree,
    r: &Ray,
    start: Start,
    entry: &mut Start,
    reqs: &mut Vec<Request>,
) -> Hit {
    let outside = start.is_none();
    let (id, b, t, p) = match start {
        Some((id, b)) => (id, b, 0.0, r.o),
        None => match enter_root(r, &tree.root_box()) {
            Some((t, p)) => match *entry {
                Some((id, b)) => (id, b, t, p),
                None => (0, tree.root_box(), t, p),
            },
            None => return Hit::miss(0),
        },
    };
    walk(tree, r, id, b, t, p, outside, entry, reqs)
}

/// The neighbour traversal of ray `r` from leaf `id` (box `b`) at distance `t` and point `p`
/// inside it (see [`crate::frustum::cast_at`]).
#[inline(always)]
pub(crate) fn walk_from(
    tree: &Octree,
    r: &Ray,
    id: u32,
    b: BoxU,
    t: f64,
    p: [f64; 3],
    reqs: &mut Vec<Request>,
) -> Hit {
    walk(tree, r, id, b, t, p, false, &mut None, reqs)
}

/// The neighbour traversal's loop, from leaf (or entry node) `id` with box `b` at distance `t`
/// and point `p`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn walk(
    tree: &Octree,
    r: &Ray,
    mut id: u32,
    mut b: BoxU,
    mut t: f64,
    mut p: [f64; 3],
    outside: bool,
    entry: &mut Start,
    reqs: &mut Vec<Request>,
) -> Hit {
    let nodes = &tree.nodes;
    let anchor = &tree.anchor;
    let mut first = outside;
    let mut last_brick = NONE;
    let lod = r.lod;
    let mut steps = 1u32;
    // Link to improve: (owner, face, owner depth, link target).
    let mut opt: Option<(u32, usize, u8, u32)> = None;
    loop {
        // Climb while the point is outside, or the parent is already below the footprint.
        loop {
            let lod_parent = b.depth > 0 && dim_at(b.depth - 1) < t * lod;
            if !lod_parent && b.contains(p) {
                break;
            }
            if b.depth == 0 {
                return Hit::miss(steps);
            }
            opt = None;
            id = nodes[id as usize].parent;
            b = anchor.parent(&b);
            steps += 1;
        }
        // Descend to the leaf, or stop early on an inner node below the footprint.
        loop {
            let n = &nodes[id as usize];
            if n.is_leaf() {
                break;
            }
            if b.dim() < t * lod {
                if first {
                    set_entry(entry, id, b.min[0], b.min[1], b.min[2], b.depth);
                }
                mark_visited(tree, id);
                return Hit {
                    t,
                    drawn: t,
                    colour: n.colour,
                    node: id,
                    steps,
                    depth: b.depth,
                };
            }
            let o = b.octant_of(p);
            id = n.children + o as u32;
            b = b.child(o);
            steps += 1;
            if let Some((owner, f, dn, _)) = opt
                && b.depth == dn
            {
                nodes[owner as usize].set_link(f, id);
                opt = None;
            }
        }
        if let Some((owner, f, dn, old)) = opt.take()
            && b.depth <= dn
            && id != old
        {
            nodes[owner as usize].set_link(f, id);
        }
        if first {
            set_entry(entry, id, b.min[0], b.min[1], b.min[2], b.depth);
            first = false;
        }
        if let Some(h) = stop_here(tree, r, id, &b, t, lod, steps, &mut last_brick, reqs) {
            return h;
        }
        if steps > MAX_STEPS {
            return Hit::miss(steps);
        }
        let (t1, f, p1) = exit(r, &b, t);
        let nb = nodes[id as usize].link(f);
        if nb == NONE {
            return Hit::miss(steps);
        }
        // `exit` clamps the exit point into the same-size box across the face, so this only
        // guards against NaN; the link's improvement is defined for points in that box.
        let nd = nodes[nb as usize].depth;
        let inside = || {
            let (axis, s) = (f >> 1, b.dim());
            (0..3).all(|a| a == axis || (p1[a] >= b.min[a] && p1[a] < b.min[a] + s))
        };
        opt = if nd < b.depth && inside() {
            Some((id, f, b.depth, nb))
        } else {
            None
        };
        b = if nd == b.depth {
            b.across(f)
        } else {
            anchor.snap(&b.across(f), nd)
        };
        id = nb;
        t = t1;
        p = p1;
        steps += 1;
    }
}

/// Records where a ray entered the root (`*entry = Some((id, box))`), from the box's fields
/// passed in registers. Written inline, the copy of the box just built on the stack by the
/// descent read it back with one wide load spanning its narrower stores, which stalls store
/// forwarding: 17 % of `cast_neighbour` in a Menger zoom (eye outside the root).
#[inline(never)]
fn set_entry(entry: &mut Start, id: u32, x: f64, y: f64, z: f64, depth: u8) {
    *entry = Some((
        id,
        BoxU {
            min: [x, y, z],
            depth,
        },
    ));
}

/// kd-restart: every leaf is found by a descent from the root.
pub fn cast_kdrestart(tree: &Octree, r: &Ray, eye_inside: bool, reqs: &mut Vec<Request>) -> Hit {
    let nodes = &tree.nodes;
    let (mut t, mut p) = if eye_inside {
        (0.0, r.o)
    } else {
        match enter_root(r, &tree.root_box()) {
            Some(x) => x,
            None => return Hit::miss(0),
        }
    };
    let root = tree.root_box();
    let lod = r.lod;
    let mut steps = 0u32;
    let mut last_brick = NONE;
    loop {
        let mut b = root;
        if !b.contains(p) {
            return Hit::miss(steps);
        }
        let mut id = 0u32;
        steps += 1;
        loop {
            let n = &nodes[id as usize];
            if n.is_leaf() {
                break;
            }
            if b.dim() < t * lod {
                mark_visited(tree, id);
                return Hit {
                    t,
                    drawn: t,
                    colour: n.colour,
                    node: id,
                    steps,
                    depth: b.depth,
                };
            }
            let o = b.octant_of(p);
            id = n.children + o as u32;
            b = b.child(o);
            steps += 1;
        }
        if let Some(h) = stop_here(tree, r, id, &b, t, lod, steps, &mut last_brick, reqs) {
            return h;
        }
        if steps > MAX_STEPS {
            return Hit::miss(steps);
        }
        let (t1, _, p1) = exit(r, &b, t);
        t = t1;
        p = p1;
    }
}
