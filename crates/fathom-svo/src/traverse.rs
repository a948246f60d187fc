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
use crate::node::{NONE, REQUESTED};
use crate::octree::{BoxU, Octree, dim_at};

/// Most node steps one ray may take before it is declared a miss (a guard, never reached on a
/// consistent tree).
pub const MAX_STEPS: u32 = 1 << 16;

/// A ray in root units.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Origin.
    pub o: [f64; 3],
    /// Unit direction.
    pub d: [f64; 3],
    /// Implicit-LOD factor: a node is below the pixel footprint when `side < t * lod`.
    pub lod: f64,
    /// `1 / d` per axis.
    pub inv: [f64; 3],
}

impl Ray {
    /// A ray from `o` along unit `d` with LOD factor `lod`.
    pub fn new(o: [f64; 3], d: [f64; 3], lod: f64) -> Ray {
        Ray {
            o,
            d,
            lod,
            inv: d.map(|x| 1.0 / x),
        }
    }
}

/// What a ray found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance in root units (`f64::INFINITY` for a miss).
    pub t: f64,
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
    fn miss(steps: u32) -> Hit {
        Hit {
            t: f64::INFINITY,
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

/// Entry distance into the root (box `root`, local units) and the point just inside it, or
/// `None` when the ray misses. Uses the ray's reciprocal direction (no divisions). Inlined:
/// returned through memory, the point's components written one by one were read back as one
/// wide load by the caller, stalling store forwarding on every ray.
#[inline(always)]
fn enter_root(r: &Ray, root: &BoxU) -> Option<(f64, [f64; 3])> {
    let mut t0 = 0.0f64;
    let mut t1 = f64::INFINITY;
    let mut axis = 3;
    for a in 0..3 {
        let (min, max) = (root.min[a], root.min[a] + 1.0);
        if r.d[a] == 0.0 {
            if r.o[a] < min || r.o[a] >= max {
                return None;
            }
            continue;
        }
        let lo = (min - r.o[a]) * r.inv[a];
        let hi = (max - r.o[a]) * r.inv[a];
        let (n, f) = if r.d[a] > 0.0 { (lo, hi) } else { (hi, lo) };
        if n > t0 {
            t0 = n;
            axis = a;
        }
        t1 = t1.min(f);
    }
    if t0 > t1 {
        return None;
    }
    // Clamp into the root like `exit` does: within an ulp of a root edge, `o + t0 d` can round
    // outside, which would turn a hit on a root face into a miss. The entry face's coordinate
    // is the face itself. Built component by component, as in `exit`: an indexed store into
    // the array, read whole when the result is returned, stalled store forwarding on every
    // ray (with the eye outside the root this function was 16 % of a Menger zoom's run).
    let c = |a: usize| {
        let hi = below(root.min[a] + 1.0);
        if a == axis {
            if r.d[a] > 0.0 { root.min[a] } else { hi }
        } else {
            clamp(r.o[a] + t0 * r.d[a], root.min[a], hi)
        }
    };
    Some((t0, [c(0), c(1), c(2)]))
}

/// `x.next_down()` for the finite box coordinates `exit` uses, without the NaN and infinity
/// checks of the general function: one integer decrement for `x > 0` (local coordinates can
/// be negative: those take the general function).
#[inline(always)]
fn below(x: f64) -> f64 {
    if x > 0.0 {
        f64::from_bits(x.to_bits() - 1)
    } else {
        x.next_down()
    }
}

/// `x.clamp(lo, hi)` without its `lo <= hi` assertion (NaN stays NaN, as with `clamp`).
#[inline(always)]
fn clamp(x: f64, lo: f64, hi: f64) -> f64 {
    let y = if x < lo { lo } else { x };
    if y > hi { hi } else { y }
}

/// Exit distance of the ray from box `b`, the exit face, and the point just across it.
#[inline(always)]
pub(crate) fn exit(r: &Ray, b: &BoxU, t: f64) -> (f64, usize, [f64; 3]) {
    let s = b.dim();
    let mut best = f64::INFINITY;
    let mut axis = 0;
    for a in 0..3 {
        let da = r.d[a];
        if da == 0.0 {
            continue;
        }
        let face = if da > 0.0 { b.min[a] + s } else { b.min[a] };
        // Multiplying by the precomputed reciprocal: both traversals do the same, so their
        // results stay identical.
        let ta = (face - r.o[a]) * r.inv[a];
        if ta < best {
            best = ta;
            axis = a;
        }
    }
    let t = best.max(t);
    let pos = r.d[axis] > 0.0;
    let face = if pos {
        b.min[axis] + s
    } else {
        below(b.min[axis])
    };
    // Built component by component (no indexed store into an array that is then read whole:
    // that stalls store forwarding in this hot loop). The other coordinates are clamped into
    // this box: at an edge the exit distance equals `t`, and `o + t d` rounded can land on the
    // far side of a face the ray already crossed; without the clamp two leaves at an edge sent
    // the ray back and forth until the step guard declared a miss (seen at zoom 1e11).
    let c = |a: usize| {
        if a == axis {
            face
        } else {
            clamp(r.o[a] + t * r.d[a], b.min[a], below(b.min[a] + s))
        }
    };
    let p = [c(0), c(1), c(2)];
    (t, 2 * axis + pos as usize, p)
}

/// The leaf (or LOD-terminating inner node) handling shared by both traversals. Returns the
/// hit when the ray stops here: a full leaf wider than the ray's pixel is met where the ray
/// meets its solid part ([`crate::plane::SurfacePlane::meet`]), and passed through when it misses it (it
/// still asks for the leaf's subdivision).
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
    let mut t_hit = t;
    if b.dim() > t * lod {
        if b.depth < tree.depth_limit() && n.claim(REQUESTED) {
            reqs.push(Request { id, b: *b, t });
        }
        if n.plane.is_some() && b.dim() > t * lod * tree.plane_px {
            t_hit = n.plane.meet(r, b, t)?;
        }
    }
    Some(Hit {
        t: t_hit,
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

/// Neighbour traversal of a pixel ray from its tile's [`BeamStart`] (see [`beam_start`]): the
/// same hit as [`cast_neighbour`] from the skip node, after fewer steps.
pub fn cast_from(tree: &Octree, r: &Ray, s: &BeamStart, reqs: &mut Vec<Request>) -> Hit {
    let mut entry = None;
    // The point only has to lie in the start leaf (the climb tests containment, and the exit
    // from the leaf depends on the distance alone): its minimum corner does.
    walk(tree, r, s.id, s.b, s.t, s.b.min, false, &mut entry, reqs)
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

/// Where the pixel rays of a tile start instead of the skip node: a leaf `id` (box `b`) that
/// every ray of the tile reaches through empty leaves, and the distance `t` at which the whole
/// tile's frustum is inside it (see [`beam_start`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BeamStart {
    /// The leaf.
    pub id: u32,
    /// Its box.
    pub b: BoxU,
    /// Distance (root units) at which the rays start in it.
    pub t: f64,
}

/// Relative slack on distances in the beam's tests: far above the few ulps by which a
/// traversal's computed distance can differ from the exact one.
const BEAM_SLACK: f64 = 1.0 / (1u64 << 40) as f64;

/// Margin (relative to the coordinates' and distances' magnitude) by which the corner rays'
/// exit points must lie inside the face a tile's rays cross: ~64 ulps, far above the rounding
/// of an exit point (an ulp or two) and of a pixel's direction against the exact combination
/// of the corners' (a few ulps of the distance).
const BEAM_MARGIN: f64 = 1.0 / (1u64 << 46) as f64;

/// Most leaves a beam walks (a guard).
const BEAM_MAX_LEAVES: u32 = 4096;

/// The conservative beam start of a tile of pixels whose corner pixels cast the rays `c` (all
/// from the eye, inside the root), walking from `from`, and the node steps the beam took.
/// `from` is the skip node (the eye's leaf at distance 0) or the start of a tile containing
/// this one (a quadrant refined from its parent tile's start: the quadrant's rays are some of
/// the parent's, so from the parent's start they walk the leaves they walk from the skip node,
/// and everything below holds from there).
///
/// The corner rays walk in lockstep from the skip node: from a leaf `K` all four must leave
/// through the same face `f`, into the same leaf `K'`, each exit point at least a margin
/// inside the part of the face `K` and `K'` share (`F`, a rectangle). Why every ray of the
/// tile then crosses from `K` into `K'` through `F` too: a pixel's direction is (up to
/// rounding) a positive combination of the corners' (the camera's unnormalised directions are
/// affine in the pixel coordinates), so the pixel ray's crossing of `F`'s plane is a convex
/// combination of the corners' crossings (central projection from the eye maps the frustum's
/// section to the convex hull of the corners'), inside `F`. By convexity of each box the pixel
/// ray's segment between two such crossings lies in the box between them: every ray of the
/// tile passes through exactly the leaves the corners walked, the margin keeping its rounded
/// exit face and point the exact ones, so its traversal from the skip node steps through them
/// in the same order.
///
/// A leaf `K` of the walk is a valid start at distance `S` (the latest corner entry into it)
/// when
/// * it and every leaf before it are empty (no ray stops there), and no LOD climb fires on
///   them: `dim_at(depth - 1) < t * lod` is false at `t = S (1 + slack)`, above any pixel's
///   entry distance (a pixel crosses a plane no later than the latest corner, since its
///   direction's component towards the plane is at least the smallest corner's and its length
///   at most 1). The test is monotone in `t` and covers every ancestor of the leaf (larger
///   sides), so neither the climb nor the descent of the traversal stops early there, and the
///   pixel ray's own climb test at the start (at `t = S`) does not fire either;
/// * `S (1 + slack) < cmin * min_i x_i`, `x_i` the corners' exit distances from `K` and `cmin`
///   a lower bound of the length of a convex combination of the corners' unit directions: a
///   pixel ray leaves `K` no earlier than `|v| min_i x_i`, so at distance `S` every pixel ray
///   is inside `K`, having entered before `S`.
///
/// Bit-identical results: the traversal leaves `K` at `max(exit, t)` with `exit` the same
/// rounded face distance whatever `t` it entered at, and both the pixel's own entry distance
/// and `S` are below `exit`, so from `K` on it computes exactly the same distances and points
/// as from the skip node, including every later LOD test (the starting `t` is never seen after
/// `K`: it cannot change which LOD node a ray stops at). Only steps and the link
/// improvements on the skipped leaves differ (any valid link gives the same image). The leaves
/// the rays would have marked visited before `K` are the beam's: it marks each leaf it leaves.
pub fn beam_start(tree: &Octree, c: &[Ray; 4], from: BeamStart) -> (BeamStart, u32) {
    let nodes = &tree.nodes;
    let anchor = &tree.anchor;
    let lod = c[0].lod;
    let (mut id, mut b) = (from.id, from.b);
    let mut best = from;
    // A lower bound of |v| for v in the convex hull of the corner directions: v . u >= min_i
    // d_i . u for the unit vector u along their sum.
    let sum: [f64; 3] = std::array::from_fn(|a| c.iter().map(|r| r.d[a]).sum());
    let len = (sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]).sqrt();
    let cmin = c
        .iter()
        .map(|r| (r.d[0] * sum[0] + r.d[1] * sum[1] + r.d[2] * sum[2]) / len)
        .fold(f64::INFINITY, f64::min)
        * (1.0 - BEAM_SLACK);
    if cmin.is_nan() || cmin <= 0.0 {
        return (best, 0);
    }
    // Every corner is inside `from`'s leaf at its distance (it is a valid start for them all).
    let mut t = [from.t; 4];
    let mut steps = 0u32;
    for _ in 0..BEAM_MAX_LEAVES {
        let n = &nodes[id as usize];
        if !n.is_leaf() || !n.is_empty() {
            break;
        }
        let s = t[0].max(t[1]).max(t[2]).max(t[3]);
        let s_hi = s * (1.0 + BEAM_SLACK);
        if b.depth > 0 && dim_at(b.depth - 1) < s_hi * lod {
            break;
        }
        let e = [
            exit(&c[0], &b, t[0]),
            exit(&c[1], &b, t[1]),
            exit(&c[2], &b, t[2]),
            exit(&c[3], &b, t[3]),
        ];
        steps += 4;
        let x_min = e[0].0.min(e[1].0).min(e[2].0).min(e[3].0);
        if s_hi < cmin * x_min {
            best = BeamStart { id, b, t: s };
        }
        let f = e[0].1;
        if e.iter().any(|x| x.1 != f) {
            break;
        }
        let nb = n.link(f);
        if nb == NONE {
            break;
        }
        // The leaf across the face at the first corner's exit point, found as the traversal
        // finds it (climb while outside, descend), without its LOD tests (the next round's).
        let p = e[0].2;
        let nd = nodes[nb as usize].depth;
        let b_nb = if nd == b.depth {
            b.across(f)
        } else {
            anchor.snap(&b.across(f), nd)
        };
        let (mut id2, mut b2) = (nb, b_nb);
        let mut lost = false;
        while !b2.contains(p) {
            if b2.depth == 0 {
                lost = true;
                break;
            }
            id2 = nodes[id2 as usize].parent;
            b2 = anchor.parent(&b2);
            steps += 1;
        }
        if lost {
            break;
        }
        while !nodes[id2 as usize].is_leaf() {
            let o = b2.octant_of(p);
            id2 = nodes[id2 as usize].children + o as u32;
            b2 = b2.child(o);
            steps += 1;
        }
        // Every corner's exit point a margin inside the shared face rectangle.
        let axis = f >> 1;
        let mag = e
            .iter()
            .map(|x| x.0 + x.2[0].abs().max(x.2[1].abs()).max(x.2[2].abs()))
            .fold(0.0, f64::max);
        let delta = mag * BEAM_MARGIN;
        let (s1, s2) = (b.dim(), b2.dim());
        let inside = (0..3).filter(|&a| a != axis).all(|a| {
            let lo = b.min[a].max(b2.min[a]) + delta;
            let hi = (b.min[a] + s1).min(b2.min[a] + s2) - delta;
            e.iter().all(|x| x.2[a] >= lo && x.2[a] <= hi)
        }) && e.iter().all(|x| b2.contains(x.2));
        if !inside {
            break;
        }
        // Every ray of the tile passes through this empty leaf: mark it as they would have.
        mark_visited(tree, id);
        id = id2;
        b = b2;
        t = [e[0].0, e[1].0, e[2].0, e[3].0];
    }
    (best, steps)
}
